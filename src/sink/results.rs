//! The records of the JSON-lines files `plot` and `report` read, typed and labelled: every curve,
//! fit and diagnosis carries the label of the run it came from (its file's name, or for a file
//! holding several runs the name of that run's input as its `summary` gives it), so overlaid
//! runs are told apart as in the seed paper's figure 2.

use serde_json::Value;

use crate::gap::DiagnosisRecord;
use crate::sink::records::{CurveRecord, FitRecord};

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
    pub summaries: Vec<Labelled<Value>>,
    pub health: Vec<Labelled<Value>>,
    pub aggregates: Vec<Labelled<Value>>,
    pub limits: Vec<Labelled<Value>>,
}

fn of_type<'a>(v: &'a Value, t: &str) -> Option<&'a Value> {
    (v.get("type").and_then(Value::as_str) == Some(t)).then_some(v)
}

fn base_name(s: &str) -> String {
    std::path::Path::new(s)
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_else(|| s.to_string())
}

impl Results {
    /// Types and labels the records. Records that do not parse as their type are skipped (a
    /// newer or older writer's), never fatal.
    pub fn from_files(files: &[ResultFile]) -> Results {
        let mut out = Results::default();
        for (fi, f) in files.iter().enumerate() {
            // A run of several units: each unit's records as one run, named by the unit.
            let (records, units) = units_as_runs(&f.records);
            // Run index -> the input named by its summary (a file holding several runs).
            let mut runs_named: Vec<(Option<usize>, String)> = records
                .iter()
                .filter_map(|v| of_type(v, "summary"))
                .filter_map(|s| {
                    let run = s.get("run").and_then(Value::as_u64).map(|r| r as usize);
                    let input = s.get("input").and_then(Value::as_str)?;
                    Some((run, base_name(input)))
                })
                .collect();
            if !units.is_empty() {
                runs_named = units
                    .into_iter()
                    .enumerate()
                    .map(|(i, n)| (Some(i), n))
                    .collect();
            }
            let several = files.len() > 1;
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
            for v in &records {
                let t = v.get("type").and_then(Value::as_str).unwrap_or("");
                let run = match v.get("run").and_then(Value::as_u64) {
                    Some(r) => {
                        current = Some(r as usize);
                        current
                    }
                    None => current,
                };
                let lab = label(run);
                let at = Labelled {
                    file: fi,
                    run,
                    label: lab.clone(),
                    rec: (),
                };
                match t {
                    "curve" => {
                        if let Ok(c) = serde_json::from_value::<CurveRecord>(v.clone()) {
                            out.curves.push(at.with(c));
                        }
                    }
                    "fit" => {
                        if let Ok(c) = serde_json::from_value::<FitRecord>(v.clone()) {
                            out.fits.push(at.with(c));
                        }
                    }
                    "diagnosis" => {
                        if let Ok(c) = serde_json::from_value::<DiagnosisRecord>(v.clone()) {
                            out.diagnoses.push(at.with(c));
                        }
                    }
                    "summary" => {
                        for l in v
                            .get("limits")
                            .and_then(Value::as_array)
                            .into_iter()
                            .flatten()
                        {
                            out.limits.push(at.with(l.clone()));
                        }
                        out.summaries.push(at.with(v.clone()));
                    }
                    "health" => out.health.push(at.with(v.clone())),
                    "aggregate" => out.aggregates.push(at.with(v.clone())),
                    _ => {}
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
        let mine: Vec<&Labelled<DiagnosisRecord>> = self
            .diagnoses
            .iter()
            .filter(|d| d.file == c.file && d.run == c.run && d.rec.channel == c.rec.channel)
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
            format!("{} [{}] \u{2014} {}", c.rec.channel, c.rec.unit, c.label)
        } else {
            format!("{} [{}]", c.rec.channel, c.rec.unit)
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
    /// From a `summary` record's `read_to_end` and `stopped_by`.
    pub fn of_summary(s: &Value) -> Completion {
        let stopped = s
            .get("stopped_by")
            .and_then(Value::as_str)
            .map(String::from);
        match (s.get("read_to_end").and_then(Value::as_bool), stopped) {
            (Some(true), _) => Completion::Complete,
            (_, Some(by)) if by.starts_with("--duration") || by == "duration" => {
                Completion::Planned(by)
            }
            (_, Some(by)) => Completion::Interrupted(by),
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
