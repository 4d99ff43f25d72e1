//! `aggregate`: run-to-run statistics (the seed paper's table 2) from the JSON lines `analyze`
//! wrote, one file per run. The statistics themselves are [`allanscope::model::aggregate`]'s.
//!
//! From each file the final `fit` record of each channel is taken (`"final": true`; a file cut
//! short without one falls back to the channel's last `fit` record, with a warning). A file that
//! holds several runs (`analyze A B C` writes a `run` index into each record) counts as those
//! runs.

use std::path::Path;

use anyhow::Result;

use super::{read_json_lines, usage, AggregateArgs};
use allanscope::model::aggregate::{aggregate_channels, RunCoefs};
use allanscope::sink::json::JsonLines;
use allanscope::sink::records::{AggregateRecord, Record};
use allanscope::sink::results::ResultFile;

pub fn run(a: &AggregateArgs) -> Result<()> {
    let mut runs: Vec<Vec<RunCoefs>> = Vec::new();
    // Each run as messages name it: its file, and its run index when the file holds several.
    let mut names: Vec<String> = Vec::new();
    for path in &a.inputs {
        if !path.is_file() {
            return Err(anyhow::Error::new(allanscope::error::UsageError::Input {
                file: path.clone(),
                line: 0,
                problem: "cannot open: no such file".into(),
            }));
        }
        let found = runs_of_file(path)?;
        if found.is_empty() {
            return Err(usage(format!(
                "{}: no `fit` record (was it written by `allanscope analyze` with a fit?)",
                path.display()
            )));
        }
        let several = found.len() > 1;
        for (run, coefs) in found {
            names.push(match run {
                Some(r) if several => format!("{} run {r}", path.display()),
                _ => path.display().to_string(),
            });
            runs.push(coefs);
        }
    }
    // Refused before the output is opened: an earlier result stays as it was.
    let aggregates = aggregate_channels(&runs).map_err(|e| unit_mismatch(&e, &names))?;
    let mut sink = match &a.out {
        Some(p) => {
            // An earlier result is refused unless --force, and replaced only at the first
            // record (sink::output).
            let mode = allanscope::sink::output::OutputMode::new(a.force, false);
            let f = allanscope::sink::output::OutputFile::open(p, mode, "aggregate --out")
                .map_err(anyhow::Error::new)?;
            JsonLines::new(Box::new(std::io::BufWriter::new(f)))
        }
        // On a terminal the table shows each run's fit as a row above the statistics.
        None => JsonLines::new(super::terminal::stdout_records_with_runs(a.json, || {
            a.inputs
                .iter()
                .filter_map(|p| {
                    Some(ResultFile {
                        name: p.file_name()?.to_string_lossy().into_owned(),
                        // Only what the rows need: fits, and summaries that name the inputs.
                        records: read_json_lines(p)
                            .ok()?
                            .into_iter()
                            .filter(|v| matches!(v["type"].as_str(), Some("fit" | "summary")))
                            .collect(),
                    })
                })
                .collect()
        })),
    };
    for agg in &aggregates {
        sink.write(&Record::from(AggregateRecord::new(agg)))?;
    }
    sink.flush()?;
    Ok(())
}

/// The usage error (exit status 2) of runs whose channel is in different units, naming the runs
/// by `names` (a file, or an input of `analyze`): the statistics would average numbers in two
/// units under one.
pub(crate) fn unit_mismatch(
    e: &allanscope::model::aggregate::UnitMismatch,
    names: &[String],
) -> anyhow::Error {
    let name = |r: usize| names.get(r).cloned().unwrap_or_else(|| format!("run {r}"));
    usage(format!(
        "{}: channel {} is in {} where {} has it in {}: the runs cannot be aggregated; analyse \
         them with one --unit",
        name(e.run),
        e.channel,
        e.unit,
        name(e.first_run),
        e.first_unit
    ))
}

/// One run's channels as read so far: (is the record final, its coefficients).
type RunSoFar = (Option<usize>, Vec<(bool, RunCoefs)>);

/// The runs in one file: per run index (absent: one run), the index and each channel's final
/// fit. A file of a run of several units (`[[unit]]`) holds one run per unit: the unit-to-unit
/// statistics.
fn runs_of_file(path: &Path) -> Result<Vec<(Option<usize>, Vec<RunCoefs>)>> {
    // A file of several units holds one run per unit (`units_as_runs`); its fit records are read
    // typed, and one that does not parse is an error.
    let (values, _) = allanscope::sink::results::units_as_runs(&read_json_lines(path)?);
    let mut records = Vec::new();
    for v in values.into_iter().filter(|v| v["type"] == "fit") {
        let r = Record::from_value(v).map_err(|e| {
            usage(format!(
                "{}: a `fit` record that does not parse: {e}",
                path.display()
            ))
        })?;
        records.extend(r);
    }
    // (run index, channel) -> (is final, coefficients), the latest record winning among equals.
    let mut runs: Vec<RunSoFar> = Vec::new();
    for rec in &records {
        let Record::Fit(fit) = rec else {
            continue;
        };
        let coefs = fit.run_coefs();
        let (run, is_final) = (fit.run, fit.r#final);
        let idx = match runs.iter().position(|(r, _)| *r == run) {
            Some(i) => i,
            None => {
                runs.push((run, Vec::new()));
                runs.len() - 1
            }
        };
        let chans = &mut runs[idx].1;
        match chans.iter_mut().find(|(_, c)| c.channel == coefs.channel) {
            Some(slot) => {
                if is_final || !slot.0 {
                    *slot = (is_final, coefs);
                }
            }
            None => chans.push((is_final, coefs)),
        }
    }
    Ok(runs
        .into_iter()
        .map(|(run, chans)| {
            let coefs = chans
                .into_iter()
                .map(|(is_final, c)| {
                    if !is_final {
                        tracing::warn!(
                            "{}{}: channel {}: no final fit record, using the last one",
                            path.display(),
                            run.map(|r| format!(" run {r}")).unwrap_or_default(),
                            c.channel
                        );
                    }
                    c
                })
                .collect();
            (run, coefs)
        })
        .collect())
}
