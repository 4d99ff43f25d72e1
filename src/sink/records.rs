//! The JSON-lines records of docs/records.md, typed: every record a run writes is a [`Record`],
//! tagged by its `type` field, and every nested object (`coef`, `datasheet`, `readouts`, `limits`,
//! the diagnosis) is a struct here or in `crate::gap::record`. Field names and units here are the
//! contract: scripts read them. Extra fields may be added; none may be renamed. The structs are
//! built from the numerical stages' results (`model`, `gap`), which know nothing of JSON.
//!
//! Reading: [`Record::from_line`] parses one line; a record of a type this version does not know
//! (written by a newer version) is `Ok(None)`, to be skipped, not an error.

use serde::{Deserialize, Deserializer, Serialize};

use crate::allan::{Curve, Stat};
use crate::gap::effects::nullable_f64;
use crate::model::aggregate::{CoefAggregate, RunCoefs};
use crate::model::fit::FitResult;
use crate::model::readout::{Readout, Readouts};
pub use crate::model::term_values::{CoefValue, Terms};
use crate::model::terms::basis;
use crate::model::units::{datasheet_factors, datasheet_units, native_units, IncrementUnit};

/// A non-finite number (an undefined edf or interval) is written as JSON `null`.
fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

/// `curve`: one statistic of one channel. Arrays are parallel, one entry per tau.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(tag = "type", rename = "curve")]
pub struct CurveRecord {
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
#[serde(tag = "type", rename = "fit")]
pub struct FitRecord {
    pub channel: String,
    pub unit: String,
    pub r#final: bool,
    pub t_data: f64,
    /// `{Q, N, B, K, R}`, each `{value, lo, hi, determined}` (docs/theory.md section 2 units).
    pub coef: CoefRecord,
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
    pub datasheet: Option<DatasheetRecord>,
    /// IEEE 952 read-outs of the AVAR curve beside the fit (model::readout): `arw`,
    /// `bias_instability`, `rrw`.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub readouts: Option<Box<ReadoutsRecord>>,
    /// Q divided by LSB/sqrt(12), where the LSB is known (the seed paper's comparison).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub q_over_lsb: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub run: Option<usize>,
}

impl FitRecord {
    /// The run's determined coefficients of this channel, for run-to-run statistics
    /// (`crate::model::aggregate`): `coef.{Q..R}.value` where `determined`.
    pub fn run_coefs(&self) -> RunCoefs {
        RunCoefs {
            channel: self.channel.clone(),
            unit: self.unit.clone(),
            values: std::array::from_fn(|i| {
                let c = self.coef.by_index(i);
                c.value.filter(|v| c.determined && v.is_finite())
            }),
        }
    }
}

/// `health`: what the decoder saw (docs/records.md): the contract's six counts first, then the
/// decoder's extra detail (`crate::frame::Health`) and what the run adds to it, in alphabetical
/// order as earlier versions wrote them. Counts a file lacks read as 0.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
#[serde(tag = "type", rename = "health", default)]
pub struct HealthRecord {
    pub frames: u64,
    pub crc_errors: u64,
    pub resyncs: u64,
    pub missing: u64,
    pub duplicates: u64,
    pub bytes_skipped: u64,
    pub bytes_accepted: u64,
    pub bytes_in: u64,
    /// `--capture` only: bytes written to the capture file, and its write error if it stopped.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub capture_bytes: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub capture_error: Option<String>,
    pub counter_breaks: u64,
    pub counter_rejects: u64,
    pub invalid_values: u64,
    pub other_messages: u64,
    /// Live sources only: frames lost in outages (silences longer than the stall limit) and the
    /// number of outages (`crate::pipeline::decode`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outage_missing: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outages: Option<u64>,
    /// A run of several units (`crate::pipeline::units`): the unit's quiet spells (live sources),
    /// and its source's error when the source failed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quiet_outages: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source_error: Option<String>,
    pub stale_frames: u64,
    /// UDP input only: datagrams dropped as repeats, given up on as too late, and put back in
    /// order (`crate::pipeline::reorder`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub udp_duplicates: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub udp_late: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub udp_reordered: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub run: Option<usize>,
}

impl HealthRecord {
    /// The record of a decoder's counts, for run `run` when several inputs are analyzed.
    pub fn new(h: &crate::frame::Health, run: Option<usize>) -> HealthRecord {
        // Destructured so that a count added to `Health` cannot be left out of the record.
        let crate::frame::Health {
            frames,
            crc_errors,
            resyncs,
            missing,
            duplicates,
            bytes_skipped,
            bytes_in,
            bytes_accepted,
            other_messages,
            invalid_values,
            counter_breaks,
            stale_frames,
            counter_rejects,
        } = *h;
        HealthRecord {
            frames,
            crc_errors,
            resyncs,
            missing,
            duplicates,
            bytes_skipped,
            bytes_accepted,
            bytes_in,
            capture_bytes: None,
            capture_error: None,
            counter_breaks,
            counter_rejects,
            invalid_values,
            other_messages,
            outage_missing: None,
            outages: None,
            quiet_outages: None,
            source_error: None,
            stale_frames,
            udp_duplicates: None,
            udp_late: None,
            udp_reordered: None,
            run,
        }
    }
}

/// `summary`: one at the end of each run.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(tag = "type", rename = "summary")]
pub struct SummaryRecord {
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
    /// Text values that were infinite or beyond `ranges::MAX_ABS_VALUE`, read as gaps (frames
    /// count theirs in `health`'s `invalid_values`).
    #[serde(skip_serializing_if = "is_zero", default)]
    pub invalid_values: u64,
    /// Text cells of analysed channels that held a word, not a number (`ERR`, `OVF`, `#N/A`),
    /// read as gaps of their channel (since session 31).
    #[serde(skip_serializing_if = "is_zero", default)]
    pub flagged_cells: u64,
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
/// not a whole number of tau0, or were too large to fill (each row then read as the next sample),
/// and the rows dropped as written twice (the same stamp and values as the row before).
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
    /// Rows that repeated the row before them, stamp and values, dropped.
    #[serde(default)]
    pub duplicates: u64,
}

/// `aggregate`: run-to-run statistics of one coefficient of one channel (the seed paper's
/// table 2).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(tag = "type", rename = "aggregate")]
pub struct AggregateRecord {
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

impl AggregateRecord {
    /// The record of one coefficient's run-to-run statistics.
    pub fn new(a: &CoefAggregate) -> AggregateRecord {
        let s = a.stats.as_ref();
        AggregateRecord {
            channel: a.channel.clone(),
            unit: a.unit.clone(),
            coef: a.coef.into(),
            n: s.map_or(0, |s| s.n),
            mean: s.map(|s| s.mean),
            sd: s.and_then(|s| s.sd),
            ci_t: s.and_then(|s| s.ci_t),
            ci_z: s.and_then(|s| s.ci_z),
        }
    }
}

/// `outage`: a unit of a run of several (`[[unit]]`) that went quiet, came back, or whose
/// source failed, while the other units went on (docs/records.md, "Several units").
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(tag = "type", rename = "outage")]
pub struct OutageRecord {
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

/// The `coef` object of the `fit` record: keys Q, N, B, K, R, each a [`CoefValue`].
pub type CoefRecord = Terms<CoefValue>;

impl CoefRecord {
    /// The fit's five coefficients.
    pub fn new(f: &FitResult) -> CoefRecord {
        let v = |i: usize| {
            let e = &f.coef[i];
            CoefValue {
                value: e.determined.then_some(e.value).and_then(finite),
                lo: finite(e.lo),
                hi: finite(e.hi),
                determined: e.determined,
            }
        };
        Terms::from_fn(v)
    }
}

/// One coefficient in datasheet units (`crate::model::units::datasheet_units`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DatasheetValue {
    /// 95% interval.
    pub hi: Option<f64>,
    pub lo: Option<f64>,
    pub unit: String,
    /// `null` where the coefficient is not determined (as in `coef`).
    pub value: Option<f64>,
}

/// The `datasheet` object of the `fit` record: Q..R, each a [`DatasheetValue`].
pub type DatasheetRecord = Terms<DatasheetValue>;

impl DatasheetRecord {
    /// The `coef` of a channel in `unit`, converted (`crate::model::units::datasheet_factors`).
    pub fn new(coef: &CoefRecord, unit: &IncrementUnit) -> DatasheetRecord {
        let f = datasheet_factors(unit);
        let names = datasheet_units(unit.kind);
        let v = |i: usize| {
            let c = coef.by_index(i);
            DatasheetValue {
                value: c.value.map(|x| x * f[i]).and_then(finite),
                lo: c.lo.map(|x| x * f[i]).and_then(finite),
                hi: c.hi.map(|x| x * f[i]).and_then(finite),
                unit: names[i].to_string(),
            }
        };
        Terms::from_fn(v)
    }
}

/// One IEEE 952 read-out as the `fit` record's `readouts` prints it (`crate::model::readout`):
/// native value and interval with the native unit, where it was read, and the same in datasheet
/// units when the channel's unit is known.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReadoutRecord {
    pub value: f64,
    #[serde(deserialize_with = "nullable_f64")]
    pub lo: f64,
    #[serde(deserialize_with = "nullable_f64")]
    pub hi: f64,
    pub unit: String,
    pub tau: f64,
    pub sigma: f64,
    #[serde(deserialize_with = "nullable_f64")]
    pub slope: f64,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub datasheet: Option<ReadoutDatasheet>,
    /// Bias instability only: the fitted flicker term's share of the fitted Allan variance at
    /// the read-out's tau, `0.4413 B^2 / AVAR_fit(tau)` (docs/theory.md section 2). The read-out
    /// is `B / sqrt(share)`: near 1 the minimum is a flicker floor and reads B; well below it
    /// the minimum is where white rate and random walk meet, and the read-out is only an upper
    /// bound on B (IEEE 952's slope method on a unit without flicker).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub flicker_share: Option<f64>,
}

/// At or above this [`ReadoutRecord::flicker_share`] the bias-instability read-out is read as the
/// flicker floor: the flicker holds at least half the variance at the minimum, and the read-out
/// is at most `1/sqrt(0.5) - 1` = 41% above B. Below it, the read-out is only an upper bound.
/// (Half, not more: the share comes from the fit, and on a 40-minute run whose true share is
/// 0.83 the fitted one was 0.59.)
pub const FLICKER_FLOOR_SHARE: f64 = 0.5;

impl ReadoutRecord {
    /// Whether this read-out is only an upper bound on B (a bias instability whose minimum the
    /// fitted flicker does not dominate, [`FLICKER_FLOOR_SHARE`]).
    pub fn is_upper_bound(&self) -> bool {
        self.flicker_share.is_some_and(|s| s < FLICKER_FLOOR_SHARE)
    }

    /// Why the read-out is only an upper bound on B, for the tables and the report: `the
    /// fitted flicker is 23% of the variance there`; `None` when it is not one.
    pub fn upper_bound_reason(&self) -> Option<String> {
        let share = self.flicker_share.filter(|_| self.is_upper_bound())?;
        Some(format!(
            "the fitted flicker is {:.0}% of the variance there",
            100.0 * share
        ))
    }
}

/// A read-out in datasheet units (the entries in the order of [`ReadoutRecord`]'s).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReadoutDatasheet {
    pub value: Option<f64>,
    #[serde(deserialize_with = "nullable_f64")]
    pub lo: f64,
    #[serde(deserialize_with = "nullable_f64")]
    pub hi: f64,
    pub unit: String,
}

/// The `readouts` object of the `fit` record: `arw`, `bias_instability`, `rrw`, each a
/// [`ReadoutRecord`] or absent.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct ReadoutsRecord {
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub arw: Option<ReadoutRecord>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub bias_instability: Option<ReadoutRecord>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub rrw: Option<ReadoutRecord>,
}

impl ReadoutsRecord {
    /// The record of a curve's read-outs for a channel in `unit`; `model_c`, the fitted
    /// `(Q^2, N^2, B^2, K^2, R^2)`, gives the bias instability's flicker share.
    pub fn new(r: &Readouts, unit: &str, model_c: Option<[f64; 5]>) -> ReadoutsRecord {
        let inc = IncrementUnit::parse(unit);
        let native = native_units(unit);
        // ARW is the N coefficient, bias instability B, RRW K (indices 1, 2, 3).
        let one = |r: &Option<Readout>, i: usize| {
            r.map(|r| ReadoutRecord {
                value: r.value,
                lo: r.lo,
                hi: r.hi,
                unit: native[i].clone(),
                tau: r.tau,
                sigma: r.sigma,
                slope: r.slope,
                datasheet: inc.map(|u| {
                    let f = datasheet_factors(&u)[i];
                    ReadoutDatasheet {
                        value: Some(r.value * f),
                        lo: r.lo * f,
                        hi: r.hi * f,
                        unit: datasheet_units(u.kind)[i].to_string(),
                    }
                }),
                flicker_share: None,
            })
        };
        let share = |tau: f64| {
            let c = model_c?;
            let b = basis(tau);
            let total: f64 = (0..5).map(|k| c[k].max(0.0) * b[k]).sum();
            (total > 0.0).then(|| c[2].max(0.0) * b[2] / total)
        };
        let mut bias_instability = one(&r.bias_instability, 2);
        if let Some(bi) = bias_instability.as_mut() {
            bi.flicker_share = share(bi.tau);
        }
        ReadoutsRecord {
            arw: one(&r.arw, 1),
            bias_instability,
            rrw: one(&r.rrw, 3),
        }
    }
}

/// Any record, written as one JSON object whose `type` names the variant (`curve`, `fit`,
/// `health`, `aggregate`, `summary`, `outage`, `diagnosis`), first in the object. In a run of
/// several units the writer adds the unit's name (`crate::sink::unit_record`).
///
/// The tag belongs to each record struct (`#[serde(tag = "type", rename = "fit")]` and so on), so
/// a struct serialized on its own is a whole record too; `Record` writes its variant as it is and
/// reads a record by its `type` ([`Record::from_line`] for a line that may be of a type this
/// version does not know).
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(untagged)]
pub enum Record {
    Curve(CurveRecord),
    Fit(Box<FitRecord>),
    Health(HealthRecord),
    Aggregate(AggregateRecord),
    Summary(SummaryRecord),
    Outage(OutageRecord),
    /// `diagnosis`: the sim-to-real gap of one channel (`crate::gap::record`).
    Diagnosis(Box<crate::gap::DiagnosisRecord>),
}

impl Record {
    /// Every `type` this version writes and reads.
    pub const TYPES: [&'static str; 7] = [
        "curve",
        "fit",
        "health",
        "aggregate",
        "summary",
        "outage",
        "diagnosis",
    ];

    /// The record's `type`.
    pub fn type_name(&self) -> &'static str {
        match self {
            Record::Curve(_) => "curve",
            Record::Fit(_) => "fit",
            Record::Health(_) => "health",
            Record::Aggregate(_) => "aggregate",
            Record::Summary(_) => "summary",
            Record::Outage(_) => "outage",
            Record::Diagnosis(_) => "diagnosis",
        }
    }

    /// The record as one JSON line (no newline).
    pub fn to_json_line(&self) -> String {
        // Serializing these plain structs cannot fail (string keys, no maps of other keys).
        serde_json::to_string(self).unwrap_or_default()
    }

    /// One JSON line read back: `Ok(None)` for an object whose `type` this version does not
    /// know (a newer writer's record: skip it); an error for anything else that does not parse,
    /// a known `type` with a field missing or mistyped included.
    pub fn from_line(line: &str) -> Result<Option<Record>, serde_json::Error> {
        let v: serde_json::Value = serde_json::from_str(line)?;
        Record::from_value(v)
    }

    /// As [`Record::from_line`], from an already parsed JSON value.
    pub fn from_value(v: serde_json::Value) -> Result<Option<Record>, serde_json::Error> {
        match v.get("type").and_then(serde_json::Value::as_str) {
            Some(t) if !Record::TYPES.contains(&t) => Ok(None),
            _ => serde_json::from_value(v).map(Some),
        }
    }
}

impl<'de> Deserialize<'de> for Record {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Record, D::Error> {
        use serde::de::Error;
        let v = serde_json::Value::deserialize(d)?;
        let ty = match v.get("type") {
            Some(serde_json::Value::String(t)) => t.clone(),
            Some(_) => return Err(D::Error::custom("`type` is not a string")),
            None => return Err(D::Error::missing_field("type")),
        };
        let err = |e: serde_json::Error| D::Error::custom(e);
        Ok(match ty.as_str() {
            "curve" => Record::Curve(serde_json::from_value(v).map_err(err)?),
            "fit" => Record::Fit(serde_json::from_value(v).map_err(err)?),
            "health" => Record::Health(serde_json::from_value(v).map_err(err)?),
            "aggregate" => Record::Aggregate(serde_json::from_value(v).map_err(err)?),
            "summary" => Record::Summary(serde_json::from_value(v).map_err(err)?),
            "outage" => Record::Outage(serde_json::from_value(v).map_err(err)?),
            "diagnosis" => Record::Diagnosis(serde_json::from_value(v).map_err(err)?),
            other => {
                return Err(D::Error::unknown_variant(other, &Record::TYPES));
            }
        })
    }
}

macro_rules! record_from {
    ($t:ty, $v:ident) => {
        impl From<$t> for Record {
            fn from(r: $t) -> Record {
                Record::$v(r.into())
            }
        }
    };
}
record_from!(CurveRecord, Curve);
record_from!(FitRecord, Fit);
record_from!(HealthRecord, Health);
record_from!(AggregateRecord, Aggregate);
record_from!(SummaryRecord, Summary);
record_from!(OutageRecord, Outage);
record_from!(crate::gap::DiagnosisRecord, Diagnosis);

#[cfg(test)]
mod tests {
    use super::*;

    fn coef_value(v: Option<f64>) -> CoefValue {
        CoefValue {
            value: v,
            lo: Some(0.5),
            hi: None,
            determined: v.is_some(),
        }
    }

    fn fit() -> FitRecord {
        let coef = CoefRecord {
            Q: coef_value(None),
            N: coef_value(Some(0.25)),
            B: coef_value(Some(0.125)),
            K: coef_value(None),
            R: coef_value(None),
        };
        let unit = IncrementUnit::parse("arcsec").unwrap();
        FitRecord {
            channel: "g4".into(),
            unit: "arcsec".into(),
            r#final: true,
            t_data: 300.0,
            datasheet: Some(DatasheetRecord::new(&coef, &unit)),
            coef,
            gof: Some(1.5),
            method: "model".into(),
            model_c: vec![0.0, 0.0625, 0.015625, 0.0, 0.0],
            readouts: None,
            q_over_lsb: None,
            run: Some(2),
        }
    }

    #[test]
    fn the_type_tag_comes_first_and_the_fit_round_trips() {
        let line = Record::from(fit()).to_json_line();
        assert!(line.starts_with(r#"{"type":"fit","channel":"g4","unit":"arcsec","final":true,"t_data":300.0,"coef":{"B":{"determined":true,"hi":null,"lo":0.5,"value":0.125},"K":{"determined":false,"#), "{line}");
        // N = 0.25 arcsec/sqrt(s) is 0.25/60 deg/sqrt(h); B = 0.125 arcsec/s is 0.125 deg/h.
        let back = Record::from_line(&line).unwrap().unwrap();
        let Record::Fit(f) = &back else {
            panic!("{back:?}")
        };
        let ds = f.datasheet.as_ref().unwrap();
        assert_eq!(ds.N.value, Some(0.25 / 60.0));
        assert_eq!(ds.N.unit, "deg/sqrt(h)");
        assert_eq!(ds.B.value, Some(0.125));
        assert_eq!(ds.get("B"), Some(&ds.B));
        assert_eq!(f.coef.get("K"), Some(&f.coef.K));
        assert_eq!(f.coef.get("X"), None);
        assert_eq!(back, Record::from(fit()));
        assert_eq!(
            f.run_coefs().values,
            [None, Some(0.25), Some(0.125), None, None]
        );
    }

    #[test]
    fn health_keys_keep_their_order() {
        let h = crate::frame::Health {
            frames: 1,
            crc_errors: 2,
            resyncs: 3,
            missing: 4,
            duplicates: 5,
            bytes_skipped: 6,
            bytes_in: 7,
            bytes_accepted: 8,
            other_messages: 9,
            invalid_values: 10,
            counter_breaks: 11,
            stale_frames: 12,
            counter_rejects: 13,
        };
        let mut r = HealthRecord::new(&h, None);
        assert_eq!(
            Record::from(r.clone()).to_json_line(),
            r#"{"type":"health","frames":1,"crc_errors":2,"resyncs":3,"missing":4,"duplicates":5,"bytes_skipped":6,"bytes_accepted":8,"bytes_in":7,"counter_breaks":11,"counter_rejects":13,"invalid_values":10,"other_messages":9,"stale_frames":12}"#
        );
        r.capture_bytes = Some(100);
        r.outages = Some(1);
        r.outage_missing = Some(250);
        r.udp_late = Some(0);
        r.run = Some(1);
        let line = Record::from(r.clone()).to_json_line();
        assert!(
            line.contains(r#""bytes_in":7,"capture_bytes":100,"counter_breaks""#),
            "{line}"
        );
        assert!(line.contains(r#""other_messages":9,"outage_missing":250,"outages":1,"stale_frames":12,"udp_late":0,"run":1}"#), "{line}");
        assert_eq!(Record::from_line(&line).unwrap(), Some(Record::Health(r)));
        // An older file's health record with the six contract counts only still reads.
        let old = r#"{"type":"health","frames":10,"crc_errors":0,"resyncs":0,"missing":1,"duplicates":0,"bytes_skipped":0}"#;
        let Some(Record::Health(o)) = Record::from_line(old).unwrap() else {
            panic!("health")
        };
        assert_eq!((o.frames, o.missing, o.bytes_in), (10, 1, 0));
    }

    #[test]
    fn unknown_types_are_skipped_and_broken_known_ones_are_errors() {
        // A newer version's record.
        let newer = r#"{"type":"thermal","channel":"g1","slope":0.1}"#;
        assert_eq!(Record::from_line(newer).unwrap(), None);
        // A known type with a field missing, no type at all, not JSON.
        assert!(Record::from_line(r#"{"type":"fit","channel":"g1"}"#).is_err());
        assert!(Record::from_line(r#"{"channel":"g1"}"#).is_err());
        assert!(Record::from_line("{not json").is_err());
        // Extra fields (a newer version's additions to a known record) are ignored.
        let mut v = serde_json::to_value(Record::from(fit())).unwrap();
        v["added_later"] = serde_json::json!([1, 2]);
        assert_eq!(Record::from_value(v).unwrap(), Some(Record::from(fit())));
    }

    #[test]
    fn a_null_readout_interval_reads_back() {
        let r = ReadoutsRecord {
            arw: Some(ReadoutRecord {
                value: 0.2,
                lo: f64::NAN,
                hi: f64::INFINITY,
                unit: "arcsec/sqrt(s)".into(),
                tau: 1.0,
                sigma: 0.2,
                slope: -0.5,
                datasheet: None,
                flicker_share: None,
            }),
            ..Default::default()
        };
        let text = serde_json::to_string(&r).unwrap();
        assert!(text.contains(r#""lo":null,"hi":null"#), "{text}");
        let back: ReadoutsRecord = serde_json::from_str(&text).unwrap();
        let a = back.arw.unwrap();
        assert!(a.lo.is_nan() && a.hi.is_nan() && a.value == 0.2);
    }
}
