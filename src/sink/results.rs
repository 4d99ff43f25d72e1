//! The records of the JSON-lines files `plot`, `report` and the terminal table read, typed and
//! labelled: every curve,
//! fit and diagnosis carries the label of the run it came from (its file's name, or for a file
//! holding several runs the name of that run's input as its `summary` gives it), so overlaid
//! runs are told apart as in the seed paper's figure 2.
//!
//! Every record is read into its struct of `crate::sink::records` (or `crate::gap::record`); a
//! record of a type this version does not know, or one that does not parse as its type (a much
//! older or newer writer's), is skipped, as [`crate::sink::records::Record::from_line`] does.
//! [`ReadRecord`] is one record read so, with the unit's name of a run of several units; the
//! terminal table keeps its records in that form and [`Results::from_read`] labels them.

use serde_json::Value;

use crate::gap::DiagnosisRecord;
use crate::model::limits::LimitResult;
use crate::sink::records::{
    AggregateRecord, CurveRecord, FitRecord, HealthRecord, Record, SummaryRecord,
};

/// One input file's records.
#[derive(Debug, Clone)]
pub struct ResultFile {
    /// The file's name (no directory).
    pub name: String,
    pub records: Vec<Value>,
}

/// A record and the run it belongs to.
#[derive(Debug, Clone)]
pub struct Labelled<T> {
    /// Which input file (index into the files given).
    pub file: usize,
    /// The `run` index inside that file, when it holds several runs.
    pub run: Option<usize>,
    /// How the run is named on plots and tables.
    pub label: String,
    pub rec: T,
}

impl Labelled<()> {
    /// The same run's label on a record.
    fn with<T>(&self, rec: T) -> Labelled<T> {
        Labelled {
            file: self.file,
            run: self.run,
            label: self.label.clone(),
            rec,
        }
    }
}

/// The records of every file, typed, in file order.
#[derive(Debug, Clone, Default)]
pub struct Results {
    pub curves: Vec<Labelled<CurveRecord>>,
    pub fits: Vec<Labelled<FitRecord>>,
    pub diagnoses: Vec<Labelled<DiagnosisRecord>>,
    pub summaries: Vec<Labelled<RunSummary>>,
    pub health: Vec<Labelled<HealthRecord>>,
    pub aggregates: Vec<Labelled<AggregateRecord>>,
    /// The limits judged in the summaries, one entry per bound.
    pub limits: Vec<Labelled<LimitResult>>,
}

/// A `summary` record read back, with how far its run's input was read ([`Completion`]: a
/// summary of a writer older than `read_to_end` does not say).
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    pub record: SummaryRecord,
    pub completion: Completion,
}

fn base_name(s: &str) -> String {
    std::path::Path::new(s)
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_else(|| s.to_string())
}

/// One record read back, typed: in its one-unit shape, with the unit's name when it came from a
/// run of several units ([`crate::sink::unit_record::untag`]). Parsed once from its line or JSON
/// object; a record of a type this version does not know, or one that does not parse as its
/// type, is no `ReadRecord` (skipped, as [`Record::from_line`] does).
#[derive(Debug, Clone)]
pub struct ReadRecord {
    /// The unit's name (`unit[i].name` of a stand config of several units).
    pub unit: Option<String>,
    pub record: Record,
    /// A `summary`'s `read_to_end` as written: `None` when absent (a writer older than it), which
    /// the typed [`SummaryRecord`] cannot tell from `false`.
    read_to_end: Option<bool>,
}

impl ReadRecord {
    /// The record of a JSON object as written.
    pub fn from_value(mut v: Value) -> Option<ReadRecord> {
        let unit = crate::sink::unit_record::untag(&mut v);
        let read_to_end = v.get("read_to_end").and_then(Value::as_bool);
        let record = Record::from_value(v).ok()??;
        Some(ReadRecord {
            unit,
            record,
            read_to_end,
        })
    }

    /// The record of one JSON line; `Err` when the line is not JSON at all, `Ok(None)` when it
    /// is JSON but not a record this version reads.
    pub fn from_line(line: &[u8]) -> Result<Option<ReadRecord>, serde_json::Error> {
        let v: Value = serde_json::from_slice(line)?;
        Ok(ReadRecord::from_value(v))
    }

    /// The record's `run` index, when it has one (several inputs of one `analyze`).
    pub fn run(&self) -> Option<usize> {
        match &self.record {
            Record::Curve(c) => c.run,
            Record::Fit(f) => f.run,
            Record::Health(h) => h.run,
            Record::Summary(s) => s.run,
            Record::Aggregate(_) | Record::Outage(_) | Record::Diagnosis(_) => None,
        }
    }
}

/// One input file's records, read typed.
#[derive(Debug, Clone, Default)]
pub struct ReadFile {
    /// The file's name (no directory).
    pub name: String,
    pub records: Vec<ReadRecord>,
}

impl ReadFile {
    /// The records of `f` that this version reads, typed.
    pub fn of(f: &ResultFile) -> ReadFile {
        ReadFile {
            name: f.name.clone(),
            records: f
                .records
                .iter()
                .filter_map(|v| ReadRecord::from_value(v.clone()))
                .collect(),
        }
    }
}

impl Results {
    /// Types and labels the records. Records that do not parse as their type are skipped (a
    /// newer or older writer's), never fatal.
    pub fn from_files(files: &[ResultFile]) -> Results {
        Results::from_read(files.iter().map(ReadFile::of).collect())
    }

    /// Labels records already read typed ([`ReadFile`]), in file order.
    pub fn from_read(files: Vec<ReadFile>) -> Results {
        let several = files.len() > 1;
        let mut out = Results::default();
        for (fi, f) in files.into_iter().enumerate() {
            // A run of several units: each unit's records as one run (its index the unit's
            // place in the file), named by the unit.
            let mut units: Vec<String> = Vec::new();
            let runs: Vec<Option<usize>> = f
                .records
                .iter()
                .map(|r| match &r.unit {
                    Some(name) => Some(match units.iter().position(|u| u == name) {
                        Some(i) => i,
                        None => {
                            units.push(name.clone());
                            units.len() - 1
                        }
                    }),
                    None => r.run(),
                })
                .collect();
            // Run index -> the input named by its summary (a file holding several runs).
            let runs_named: Vec<(Option<usize>, String)> = if units.is_empty() {
                f.records
                    .iter()
                    .zip(&runs)
                    .filter_map(|(r, run)| match &r.record {
                        Record::Summary(s) => Some((*run, base_name(&s.input))),
                        _ => None,
                    })
                    .collect()
            } else {
                units
                    .into_iter()
                    .enumerate()
                    .map(|(i, n)| (Some(i), n))
                    .collect()
            };
            let label = |run: Option<usize>| -> String {
                match run {
                    Some(r) => {
                        let input = runs_named
                            .iter()
                            .find(|(x, _)| *x == Some(r))
                            .map(|(_, n)| n.clone())
                            .unwrap_or_else(|| format!("run {}", r + 1));
                        if several {
                            format!("{} / {input}", f.name)
                        } else {
                            input
                        }
                    }
                    None => f.name.clone(),
                }
            };
            // A record without a `run` index in a file of several runs (the diagnosis record
            // has none) belongs to the run of the indexed record before it: `analyze` writes
            // each run's records together.
            let mut current: Option<usize> = None;
            for (r, indexed) in f.records.into_iter().zip(runs) {
                if indexed.is_some() {
                    current = indexed;
                }
                let at = Labelled {
                    file: fi,
                    run: current,
                    label: label(current),
                    rec: (),
                };
                match r.record {
                    Record::Curve(c) => out.curves.push(at.with(c)),
                    Record::Fit(c) => out.fits.push(at.with(*c)),
                    Record::Diagnosis(c) => out.diagnoses.push(at.with(*c)),
                    Record::Summary(record) => {
                        for l in &record.limits {
                            out.limits.push(at.with(l.clone()));
                        }
                        let completion =
                            Completion::of(r.read_to_end, record.stopped_by.as_deref());
                        out.summaries
                            .push(at.with(RunSummary { record, completion }));
                    }
                    Record::Health(c) => out.health.push(at.with(c)),
                    Record::Aggregate(c) => out.aggregates.push(at.with(c)),
                    Record::Outage(_) => {}
                }
            }
        }
        out
    }

    /// The final fit of a curve's channel in the same run, if any.
    pub fn fit_of(&self, c: &Labelled<CurveRecord>) -> Option<&FitRecord> {
        self.fits
            .iter()
            .filter(|f| f.file == c.file && f.run == c.run && f.rec.channel == c.rec.channel)
            .filter(|f| f.rec.r#final)
            .map(|f| &f.rec)
            .next_back()
    }

    /// The final diagnosis of a curve's channel in the same run, if any (the last one written
    /// when none is marked final).
    pub fn diagnosis_of(&self, c: &Labelled<CurveRecord>) -> Option<&DiagnosisRecord> {
        self.diagnosis_in((c.file, c.run), &c.rec.channel)
    }

    /// The final diagnosis of `channel` in the run `(file, run index)`, if any (the last one
    /// written when none is marked final).
    pub fn diagnosis_in(
        &self,
        run: (usize, Option<usize>),
        channel: &str,
    ) -> Option<&DiagnosisRecord> {
        let mine: Vec<&Labelled<DiagnosisRecord>> = self
            .diagnoses
            .iter()
            .filter(|d| (d.file, d.run) == run && d.rec.channel == channel)
            .collect();
        mine.iter()
            .rev()
            .find(|d| d.rec.is_final)
            .or(mine.last())
            .map(|d| &d.rec)
    }

    /// Every record (interim and final) of the same curve as `c`: same run, channel and
    /// statistic, in the order written; the dynamic Allan view reads its windows from these.
    pub fn history_of<'a>(&'a self, c: &Labelled<CurveRecord>) -> Vec<&'a CurveRecord> {
        self.curves
            .iter()
            .filter(|x| {
                x.file == c.file
                    && x.run == c.run
                    && x.rec.channel == c.rec.channel
                    && x.rec.stat == c.rec.stat
            })
            .map(|x| &x.rec)
            .collect()
    }

    /// A curve's caption: channel and unit, with the run's label when there are several runs.
    pub fn curve_caption(&self, c: &Labelled<CurveRecord>) -> String {
        if self.several_runs() {
            format!(
                "{} \u{2014} {}",
                super::channel_with_unit(&c.rec.channel, &c.rec.unit),
                c.label
            )
        } else {
            super::channel_with_unit(&c.rec.channel, &c.rec.unit)
        }
    }

    /// Whether the records span several runs (files, or run indices inside a file).
    pub fn several_runs(&self) -> bool {
        let mut runs: Vec<(usize, Option<usize>)> =
            self.curves.iter().map(|c| (c.file, c.run)).collect();
        runs.extend(self.fits.iter().map(|c| (c.file, c.run)));
        runs.sort_unstable();
        runs.dedup();
        runs.len() > 1
    }
}

/// The records of a run of several units ([`crate::sink::unit_record`]) in their one-unit
/// shape, each unit's as one run (its `run` index the unit's place in the file), and the units'
/// names in that order; a file of one unit is returned as it is, with no names.
pub fn units_as_runs(records: &[Value]) -> (Vec<Value>, Vec<String>) {
    let mut units: Vec<String> = Vec::new();
    let mut out = records.to_vec();
    for v in &mut out {
        if let Some(name) = crate::sink::unit_record::untag(v) {
            let i = match units.iter().position(|u| *u == name) {
                Some(i) => i,
                None => {
                    units.push(name);
                    units.len() - 1
                }
            };
            if let Some(o) = v.as_object_mut() {
                o.insert("run".into(), i.into());
            }
        }
    }
    (out, units)
}

/// How far the input of a run was read, from its `summary` (CONTRACT.md: the summary says
/// whether the input was read to its end).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Completion {
    /// Read to its end.
    Complete,
    /// A live run ended by its `--duration`: complete as planned.
    Planned(String),
    /// Stopped early by a signal (`SIGINT`, `SIGTERM`).
    Interrupted(String),
    /// Not read to its end, for no stated reason.
    Incomplete,
    /// The summary does not say (an older writer).
    Unknown,
}

impl Completion {
    /// From a `summary` record's `read_to_end` (absent from an older writer's) and `stopped_by`.
    pub fn of(read_to_end: Option<bool>, stopped_by: Option<&str>) -> Completion {
        match (read_to_end, stopped_by) {
            (Some(true), _) => Completion::Complete,
            (_, Some(by)) if by.starts_with("--duration") || by == "duration" => {
                Completion::Planned(by.to_string())
            }
            (_, Some(by)) => Completion::Interrupted(by.to_string()),
            (Some(false), None) => Completion::Incomplete,
            (None, None) => Completion::Unknown,
        }
    }

    /// Whether a person must be warned.
    pub fn is_warning(&self) -> bool {
        matches!(self, Completion::Interrupted(_) | Completion::Incomplete)
    }

    /// A short phrase for tables.
    pub fn phrase(&self) -> String {
        match self {
            Completion::Complete => "read to its end".into(),
            Completion::Planned(by) => format!("live run, ended by {by}"),
            Completion::Interrupted(by) => format!("INTERRUPTED ({by}): input not read to its end"),
            Completion::Incomplete => "INCOMPLETE: input not read to its end".into(),
            Completion::Unknown => "not stated".into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::limits::{Scope, Verdict};
    use serde_json::json;

    fn summary(extra: Value) -> Value {
        let mut s = json!({"type": "summary", "input": "runs/a.csv", "channels": ["g4"],
            "tau0": 0.004, "t_data": 60.0, "samples": [15000], "segments": [1], "bad_rows": 0,
            "overlap": "16", "elapsed_s": 0.5,
            "limits": [{"bound": "max", "channel": "g4", "coef": "N", "hi": 0.26, "limit": 0.3,
                "lo": 0.25, "over": "runs_sd", "unit": "native", "value": 0.255,
                "verdict": "pass"}]});
        for (k, v) in extra.as_object().unwrap() {
            s[k] = v.clone();
        }
        s
    }

    #[test]
    fn summaries_limits_and_health_are_read_typed() {
        let file = ResultFile {
            name: "a.jsonl".into(),
            records: vec![
                summary(json!({"read_to_end": false, "stopped_by": "SIGINT"})),
                json!({"type": "health", "frames": 7, "missing": 2}),
                json!({"type": "aggregate", "channel": "g4", "unit": "arcsec", "coef": "N",
                    "n": 3, "mean": 0.25, "sd": null, "ci_t": null, "ci_z": [0.2, 0.3]}),
                // A newer writer's record type, and a summary that is not one: skipped.
                json!({"type": "vibration", "channel": "g4"}),
                json!({"type": "summary", "input": 3}),
            ],
        };
        let res = Results::from_files(&[file]);
        assert_eq!(res.summaries.len(), 1);
        let s = &res.summaries[0].rec;
        assert_eq!(s.record.channels, ["g4"]);
        assert_eq!(s.completion, Completion::Interrupted("SIGINT".into()));
        assert_eq!(res.limits.len(), 1);
        let l = &res.limits[0].rec;
        assert_eq!(
            (l.over, l.verdict, l.value),
            (Scope::RunsSd, Verdict::Pass, Some(0.255))
        );
        assert_eq!(res.health[0].rec.frames, 7);
        assert_eq!(res.health[0].rec.missing, 2);
        // A count the health record lacks reads as 0.
        assert_eq!(res.health[0].rec.crc_errors, 0);
        assert_eq!(res.aggregates[0].rec.ci_z, Some([0.2, 0.3]));
        assert_eq!(res.aggregates[0].rec.sd, None);
    }

    /// A summary of a writer older than `read_to_end` does not say how far it read; one that
    /// says so is complete, or stopped, or incomplete.
    #[test]
    fn completion_follows_read_to_end_and_stopped_by() {
        let of = |extra: Value| {
            let res = Results::from_files(&[ResultFile {
                name: "a".into(),
                records: vec![summary(extra)],
            }]);
            res.summaries[0].rec.completion.clone()
        };
        assert_eq!(of(json!({})), Completion::Unknown);
        assert_eq!(of(json!({"read_to_end": true})), Completion::Complete);
        assert_eq!(of(json!({"read_to_end": false})), Completion::Incomplete);
        assert_eq!(
            of(json!({"read_to_end": false, "stopped_by": "--duration"})),
            Completion::Planned("--duration".into())
        );
    }

    /// The names the tables print are the names the records write.
    #[test]
    fn limit_names_are_the_record_names() {
        for v in [
            Verdict::Pass,
            Verdict::Fail,
            Verdict::Undecided,
            Verdict::Invalid,
        ] {
            assert_eq!(serde_json::to_value(v).unwrap(), v.name());
        }
        for o in [Scope::Run, Scope::RunsSd, Scope::RunsMean] {
            assert_eq!(serde_json::to_value(o).unwrap(), o.name());
        }
    }
}
